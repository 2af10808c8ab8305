//! POV-Ray 3.7 as the peer of `quadray bench images`: one render of a `.pov` file with given
//! anti-aliasing options, its image and the CPU time of its trace phase, and the measurement of
//! every anti-aliasing setting against POV-Ray's own converged image.

use super::{ImagesArgs, Method, POV_CHECK_SCALE, POV_REFERENCE_SCALE, PovReport, Row};
use crate::compare::{LinearImage, Thresholds, compare, read_image};
use anyhow::{Context, Result, bail};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// One POV-Ray render.
pub struct PovRender {
    /// The 8-bit sRGB image it wrote.
    pub image: LinearImage,
    /// CPU seconds of its "Trace Time" (parsing and bounding excluded, like quadray's BVH build).
    pub trace_cpu: f64,
}

/// POV-Ray's converged image, then each anti-aliasing setting `runs` times against it.
pub fn measure(a: &ImagesArgs, pov: &Path, progress: &mut dyn FnMut(&str)) -> Result<PovReport> {
    let scratch = a
        .out
        .join(format!(".{}-povray-{}.png", a.name, std::process::id()));
    progress(&format!(
        "POV-Ray reference: {} at {POV_REFERENCE_SCALE}x the resolution",
        a.pov_reference
    ));
    let reference = render_scaled(pov, a.res, POV_REFERENCE_SCALE, &a.pov_reference, &scratch)?;
    let reference_check = if a.no_reference_check {
        None
    } else {
        progress(&format!(
            "second POV-Ray reference: {} at {POV_CHECK_SCALE}x the resolution",
            a.pov_reference
        ));
        let check = render_scaled(pov, a.res, POV_CHECK_SCALE, &a.pov_reference, &scratch)?;
        let between = compare(&reference.image, &check.image, &Thresholds::default())?;
        Some(between.rmse_display)
    };
    let mut rows = Vec::new();
    for options in &a.pov_aa {
        progress(&format!("POV-Ray {options}, {} runs", a.runs));
        let (mut wall, mut cpu, mut last) = (Vec::new(), Vec::new(), None);
        for _ in 0..a.runs {
            let start = Instant::now();
            let run = render(pov, a.res, options, &scratch)?;
            wall.push(start.elapsed().as_secs_f64());
            cpu.push(run.trace_cpu);
            last = Some(run.image);
        }
        let image = last.context("no POV-Ray run")?;
        rows.push(Row {
            method: Method::PovRay(options.clone()),
            wall,
            cpu,
            rays: None,
            sampling: None,
            error: compare(&reference.image, &image, &Thresholds::default())?,
        });
    }
    Ok(PovReport {
        file: pov.to_path_buf(),
        reference_options: a.pov_reference.clone(),
        reference_cpu: reference.trace_cpu,
        reference_check,
        rows,
    })
}

/// Renders `pov` at `scale` times `width` × `height` with `options` and averages each
/// `scale` × `scale` block of linear pixels into one: the pixel's box integral, as quadray's
/// samples estimate it.
pub fn render_scaled(
    pov: &Path,
    (width, height): (u32, u32),
    scale: u32,
    options: &str,
    scratch: &Path,
) -> Result<PovRender> {
    let fine = render(pov, (width * scale, height * scale), options, scratch)?;
    Ok(PovRender {
        image: box_down(&fine.image, scale),
        trace_cpu: fine.trace_cpu,
    })
}

/// `image` averaged over blocks of `scale` × `scale` pixels (its size a multiple of `scale`).
fn box_down(image: &LinearImage, scale: u32) -> LinearImage {
    let (width, height) = (image.width / scale, image.height / scale);
    let area = (scale * scale) as f32;
    let pixels = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let mut sum = [0.0f32; 3];
            for dy in 0..scale {
                let row = (y * scale + dy) * image.width;
                for dx in 0..scale {
                    let p = image.pixels[(row + x * scale + dx) as usize];
                    for c in 0..3 {
                        sum[c] += p[c];
                    }
                }
            }
            sum.map(|v| v / area)
        })
        .collect();
    LinearImage {
        width,
        height,
        pixels,
    }
}

/// Renders `pov` at `width` × `height` on one thread with `options` (e.g. `+A0.1 +AM2 +R3`, or
/// `-A`), writing its PNG to `scratch` (removed afterwards).
pub fn render(
    pov: &Path,
    (width, height): (u32, u32),
    options: &str,
    scratch: &Path,
) -> Result<PovRender> {
    let dir = pov
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let file = pov.file_name().context("the .pov path names no file")?;
    let scratch = std::path::absolute(scratch)?;
    let output = Command::new("povray")
        .current_dir(dir)
        .arg(format!("+I{}", file.to_string_lossy()))
        .arg(format!("+O{}", scratch.display()))
        .args([format!("+W{width}"), format!("+H{height}")])
        // Headless, quiet, PNG with the sRGB curve, one render thread.
        .args(["-D", "-V", "+FN", "File_Gamma=sRGB", "+WT1"])
        .args(options.split_whitespace())
        .output()
        .context("running povray (apt-get install povray)")?;
    let log = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        bail!(
            "povray {} {options} failed ({}): {}",
            pov.display(),
            output.status,
            log.lines().rev().take(5).collect::<Vec<_>>().join(" / ")
        );
    }
    let trace_cpu = trace_cpu_seconds(&log)
        .with_context(|| format!("no trace time in povray's statistics for {}", pov.display()))?;
    let image = read_image(&scratch);
    let _ = std::fs::remove_file(&scratch);
    Ok(PovRender {
        image: image?,
        trace_cpu,
    })
}

/// The CPU seconds on the line after "Trace Time:" in POV-Ray's statistics
/// (`using 1 thread(s) with 0.341 CPU-seconds total`).
fn trace_cpu_seconds(log: &str) -> Option<f64> {
    let mut lines = log
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("Trace Time:"));
    lines.next()?;
    let usage = lines.next()?;
    let before = usage.split("CPU-seconds").next()?;
    before.split_whitespace().last()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Averaging blocks keeps a flat image and halves a two-pixel ramp's blocks to their mean.
    #[test]
    fn box_down_averages_blocks() {
        let image = LinearImage {
            width: 4,
            height: 2,
            pixels: (0..8).map(|i| [i as f32, 1.0, 0.5]).collect(),
        };
        let down = box_down(&image, 2);
        assert_eq!((down.width, down.height), (2, 1));
        // Block (0, 0) holds pixels 0, 1, 4, 5; block (1, 0) holds 2, 3, 6, 7.
        assert_eq!(down.pixels, vec![[2.5, 1.0, 0.5], [4.5, 1.0, 0.5]]);
    }

    #[test]
    fn the_trace_cpu_time_is_read_from_the_statistics() {
        let log = "Render Time:\n  Photon Time:      No photons\n  Trace Time:       0 hours  0 minutes  0 seconds (0.342 seconds)\n              using 1 thread(s) with 0.341 CPU-seconds total\n";
        assert_eq!(trace_cpu_seconds(log), Some(0.341));
        assert_eq!(
            trace_cpu_seconds("Parse Time: 1\nusing 1 thread(s) with 2.0 CPU-seconds total"),
            None
        );
    }
}
